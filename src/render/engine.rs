//! Which engine renders a scene: the user's request (`render.engine`, a
//! [`crate::scene::EngineChoice`]) checked against what each engine can address, or under
//! `auto` the cheapest exact enough for the view, with the reason in words for `--stats`.
//!
//! The policy lives with the renderer, not the scene: the scene keeps what the user asked
//! for; a render computes its [`EnginePlan`] once ([`plan`]) and hands it down to the field
//! preparation, the deep engine and the statistics. Messages name the scene setting
//! (`render.engine`); the command line adds its flag.

use crate::formula::Formula;
use crate::gpu::{self, Precision};
use crate::orbit::Numbers;
use crate::orbit::interior::Detection;
use crate::scene::{EngineChoice, FamilySpec, Scene};

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
        "the view is too deep for the f64 engine: at zoom 1e{log10_zoom:.1} a sample spans only {ulps:.3e} f64 ulps of the coordinates (at least {F64_MIN_ULPS_PER_PIXEL} are needed); set render.engine to \"auto\", \"perturb-f64\" or \"perturb-floatexp\""
    )]
    F64TooDeep {
        /// log10 of the zoom.
        log10_zoom: f64,
        /// f64 ulps per sample.
        ulps: f64,
    },
    /// `--engine perturb-f64` where f64 deltas underflow.
    #[error(
        "the view is too deep for perturbation with f64 deltas: the sample spacing 1e{log10_spacing:.1} is below 1e{min_log10_spacing}, where f64 deltas underflow; set render.engine to \"auto\" or \"perturb-floatexp\""
    )]
    DeltasUnderflow {
        /// log10 of the sample spacing.
        log10_spacing: f64,
        /// The smallest spacing f64 deltas take.
        min_log10_spacing: f64,
    },
    /// A GPU engine on a formula other than z² + c.
    #[error(
        "render.engine = \"{engine}\": the GPU paths draw z^2 + c only, not {formula}; set it to \"auto\" or \"f64\""
    )]
    GpuFormula {
        /// The engine's name.
        engine: &'static str,
        /// The scene's formula.
        formula: String,
    },
    /// Interior detection requested for a formula it does not serve.
    #[error(
        "render.interior_detection = true: interior detection (attracting cycles by Newton's method on the quadratic model of a minibrot) is built for z^2 + c only, not {formula}; remove the key or set it to false"
    )]
    InteriorFormula {
        /// The scene's formula.
        formula: String,
    },
    /// A GPU engine cannot draw the scene's traps.
    #[error("render.engine = \"{engine}\": {reason}; set it to \"auto\"")]
    GpuTraps {
        /// The engine's name.
        engine: &'static str,
        /// What the GPU paths lack.
        reason: String,
    },
    /// The GPU paths draw unrotated, unstretched views only.
    #[error(
        "render.engine = \"{engine}\": the GPU paths draw only flat views without rotation or stretch (view.rotate, view.stretch_amount, view.exponential_map); set it to \"auto\""
    )]
    GpuTransform {
        /// The engine's name.
        engine: &'static str,
    },
    /// A GPU engine's escape radius limit.
    #[error(
        "render.engine = \"{engine}\": iteration.escape_radius = {escape_radius:e} is above the GPU's limit of 2^60 (|z|^2 must stay finite in f32)"
    )]
    GpuEscapeRadius {
        /// The engine's name.
        engine: &'static str,
        /// The scene's escape radius.
        escape_radius: f64,
    },
    /// A GPU engine on a view past the f64 range.
    #[error(
        "render.engine = \"{engine}\": the view is too deep for direct iteration (zoom 1e{log10_zoom:.1} is past the f64 range); set it to \"auto\""
    )]
    GpuPastF64 {
        /// The engine's name.
        engine: &'static str,
        /// log10 of the zoom.
        log10_zoom: f64,
    },
    /// A GPU engine on a view deeper than its precision resolves.
    #[error(
        "render.engine = \"{engine}\": the view is too deep for {precision}: at zoom 1e{log10_zoom:.1} neighbouring samples are {ulps:.2} rounding units apart (at least 1 is needed); set it to {better}"
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

/// The smallest sample spacing (log10) f64 deltas take in a Julia form: the rebased step
/// is δ -> f(δ) with nothing added, and δ^p must stay a normal f64 for deltas down to the
/// spacing (p the largest power of the formula's phases).
fn julia_min_spacing(formula: &Formula) -> f64 {
    let p = formula.phases().iter().map(|p| p.power).max().unwrap_or(2);
    PERTURB_F64_MIN_LOG10_SPACING_JULIA * 2.0 / p as f64
}

/// Chooses the engine for `scene`'s view (or checks the one its `render.engine` forces),
/// and says why. A render computes this once and hands it down.
pub fn plan(scene: &Scene) -> Result<EnginePlan, EngineError> {
    plan_for(scene, scene.engine)
}

/// Like [`plan`] for a given choice (`compare` measures several on one scene).
pub fn plan_for(scene: &Scene, choice: EngineChoice) -> Result<EnginePlan, EngineError> {
    let ulps = scene.ulps_per_sample();
    let depth = -scene.log10_radius + 2f64.log10();
    let spacing = scene.log10_spacing();
    let f64_ok = ulps >= F64_MIN_ULPS_PER_PIXEL;
    let f64_exact = f64_ok && depth <= F64_AUTO_MAX_LOG10_ZOOM;
    if !scene.formula.is_quadratic() && scene.interior_detection == Detection::On {
        return Err(EngineError::InteriorFormula { formula: scene.formula.to_string() });
    }
    let min_spacing = match scene.family {
        FamilySpec::Mandelbrot => PERTURB_F64_MIN_LOG10_SPACING,
        FamilySpec::Julia { .. } => julia_min_spacing(&scene.formula),
    };
    let deltas_ok = spacing > min_spacing;
    let bla = if scene.traps.iter().all(|t| !t.observes_orbit()) { scene.bla } else { None };
    let bla_note = match (scene.bla, bla) {
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
                    "zoom 1e{depth:.1} is past 1e{F64_AUTO_MAX_LOG10_ZOOM}, where direct f64's rounding starts to show in the smooth iteration (the f64 engine still renders it, faster and less exact), so perturbation with f64 deltas{bla_note}"
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
        EngineChoice::Gpu => gpu_plan(scene, Precision::F32),
        EngineChoice::GpuDf => gpu_plan(scene, Precision::DoubleFloat),
    }
}

/// The GPU engine in `precision`, or why it cannot address the scene: traps other than
/// one bitmap trap, the stripe average, a rotated or stretched view, an escape radius past 2^60, a view past the f64
/// range, or a view deeper than the precision resolves ([`Precision::exhausted`]).
fn gpu_plan(scene: &Scene, precision: Precision) -> Result<EnginePlan, EngineError> {
    let name = precision.name();
    if !scene.formula.is_quadratic() {
        return Err(EngineError::GpuFormula { engine: name, formula: scene.formula.to_string() });
    }
    gpu::field::supported_trap(&scene.traps)
        .map_err(|e| EngineError::GpuTraps { engine: name, reason: e.to_string() })?;
    if !scene.transform.is_identity() || !scene.projection.is_flat() {
        return Err(EngineError::GpuTransform { engine: name });
    }
    if scene.escape_radius > gpu::MAX_ESCAPE_RADIUS {
        return Err(EngineError::GpuEscapeRadius { engine: name, escape_radius: scene.escape_radius });
    }
    let depth = -scene.log10_radius + 2f64.log10();
    let spacing = 2.0 * scene.radius / (scene.height * scene.aa) as f64;
    if !(scene.radius.is_normal() && spacing.is_normal()) {
        return Err(EngineError::GpuPastF64 { engine: name, log10_zoom: depth });
    }
    let center = scene.center_f64();
    let ulps = precision.ulps_per_sample(spacing, center);
    if precision.exhausted(spacing, center) {
        let better = match precision {
            Precision::F32 => "\"gpu-df\", \"f64\" or \"auto\"",
            Precision::DoubleFloat => "\"auto\"",
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
        reason: if ulps >= gpu::AGREEMENT_ULPS {
            format!("forced; a sample spans {ulps:.3e} {} rounding units", precision.describe())
        } else {
            format!(
                "forced; a sample spans only {ulps:.3e} {} rounding units: below ~{} expect N to differ from exact \
                 arithmetic on more than 1% of pixels near the boundary",
                precision.describe(),
                gpu::AGREEMENT_ULPS
            )
        },
    })
}
