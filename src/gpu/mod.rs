//! GPU paths: WGSL versions of the 2D escape-time field and the IFS density field, run
//! through wgpu.
//!
//! The GPU computes the same per-sample quantities as [`crate::field`] (N, NF, T,
//! DEX/DEY, a bitmap trap's colour) for views that 24-bit floats can address, in two
//! precisions ([`Precision`]): plain f32, which is what a GPU does fast, and double-float
//! (an unevaluated sum of two f32s, about 46 bits), which reaches roughly 10^7 times
//! deeper at a fraction of the speed. Neither replaces the f64 or perturbation engines:
//! renders use the GPU only when asked (`--engine gpu` or `gpu-df`), and `auto` never
//! picks it. The viewer draws with it (its paint callback, `src/viewer/paint.rs`, which
//! appends a fragment shader to [`shaders::escape_module`]) because it is interactive at
//! any size. Nothing here knows egui or eframe.
//!
//! * [`GpuContext`]: a headless device (any backend, a software rasteriser such as
//!   lavapipe included) and the compute pipelines, built once and cached.
//! * [`uniforms`]: the single uniform block all pipelines share.
//! * [`shaders`]: the WGSL text and how modules are assembled from shared pieces.
//! * [`field`]: raw planes of a strip of the sample grid ([`field::compute_planes`]).
//! * [`ifs`]: the minimal IFS density field (p ← abs(p)/dot(p,p) + offset), on the CPU and on the GPU.
//! * `runner`: chunked compute dispatches with readback.
//!
//! Everything that opens a device (the context, the runner, [`ifs`]'s dispatch) is
//! compiled only with the `gpu` cargo feature, on by default; the precisions, limits and
//! shader text are always here, so scenes
//! and `--engine` parse the same in a headless build, which refuses the GPU engines with
//! [`GpuError::NotBuilt`].
//!
//! The GPU owns no maths types: planes come back as the same [`crate::field::Planes`] the
//! CPU kernels fill, and the rest of the program (colouring, files) cannot tell them apart.

#[cfg(not(feature = "gpu"))]
mod absent;
#[cfg(feature = "gpu")]
mod context;
pub mod field;
#[cfg(feature = "gpu")]
pub mod ifs;
#[cfg(feature = "gpu")]
mod runner;
pub mod shaders;
pub mod uniforms;

#[cfg(not(feature = "gpu"))]
pub use absent::GpuContext;
#[cfg(feature = "gpu")]
pub use context::GpuContext;
// For the viewer's paint callback, which builds its render pipelines on this device code.
#[cfg(feature = "viewer")]
pub(crate) use context::{checked, uniform_entry};
#[cfg(feature = "viewer")]
pub(crate) use runner::read_back;

/// Arithmetic of the GPU orbit loop.
///
/// A precision stops resolving a pixel when the spacing between samples falls below the
/// rounding unit of the coordinates, ulp ≈ `relative_ulp` × max(|centre|, 1)
/// ([`Precision::exhausted`]: neighbouring samples are then the same number). At
/// |centre| ≈ 1 and 1080 rows:
///
/// * [`Precision::F32`]: 24-bit significands, relative ulp 2^-23 ≈ 1.2e-7; exhausted past
///   zoom ≈ 3e4 (1e5 at 300 rows).
/// * [`Precision::DoubleFloat`]: hi + lo with 24 bits each, about 2^-46 ≈ 1.4e-14 relative
///   after the additions' roundings; exhausted past zoom ≈ 3e11 (1e12 at 300 rows). (Views
///   centred on short binary fractions, such as c = i, go deeper: the low parts then hold
///   the offsets exactly, as perturbation would.)
///
/// The picture degrades long before that, as the orbit amplifies rounding near the
/// boundary. `tests/integration/gpu.rs` measures, against the perturbation engine on a
/// 64x48 view of a Misiurewicz point, that N agrees on at least 99% of pixels down to
/// about [`AGREEMENT_ULPS`] rounding units per sample: zoom 1e3 in f32 and 1e10 in
/// double-float at 48 rows, i.e. about 50 and 5e8 at 1080 rows (the f64 engine, for
/// comparison, is refused below 1024 of its own ulps, past zoom ≈ 1e11 at 1080 rows).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Precision {
    /// Plain f32 arithmetic.
    F32,
    /// Double-float: each coordinate of z and c is an unevaluated sum of two f32s.
    DoubleFloat,
}

impl Precision {
    /// The engine name (`gpu`, `gpu-df`).
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "gpu",
            Precision::DoubleFloat => "gpu-df",
        }
    }

    /// What `--stats` prints as the precision.
    pub fn describe(self) -> &'static str {
        match self {
            Precision::F32 => "GPU f32",
            Precision::DoubleFloat => "GPU double-float (two f32)",
        }
    }

    /// Rounding unit of a coordinate relative to its magnitude.
    pub fn relative_ulp(self) -> f64 {
        match self {
            Precision::F32 => 2f64.powi(-23),
            Precision::DoubleFloat => 2f64.powi(-46),
        }
    }

    /// Rounding units of the coordinates per sample spacing at a view centred on `center`
    /// (magnitudes below 1 count as 1: orbits meet values of size ~1 whatever the view).
    pub fn ulps_per_sample(self, spacing: f64, center: [f64; 2]) -> f64 {
        let magnitude = center[0].abs().max(center[1].abs()).max(1.0);
        spacing / (self.relative_ulp() * magnitude)
    }

    /// True when neighbouring samples at this spacing are no longer distinct numbers in
    /// this precision (less than one rounding unit apart), or the spacing is not a normal,
    /// positive number f32 can hold (the double-float's low part must be representable).
    pub fn exhausted(self, spacing: f64, center: [f64; 2]) -> bool {
        if !(spacing.is_finite() && spacing > 1e-30 && spacing < 1e30) {
            return true;
        }
        let ulps = self.ulps_per_sample(spacing, center);
        ulps.is_nan() || ulps < 1.0
    }
}

/// Rounding units per sample below which N stops agreeing with exact arithmetic on 99% of
/// pixels (measured at a Misiurewicz point, both precisions: 590 to 700 suffice, 60 to 70
/// do not; see [`Precision`]).
pub const AGREEMENT_ULPS: f64 = 600.0;

/// Largest escape radius the GPU accepts: z_n^2 must stay finite in f32 (2^120 < 2^128).
pub const MAX_ESCAPE_RADIUS: f64 = 1.152_921_504_606_847e18; // 2^60

/// What went wrong on the GPU side.
#[derive(Debug, Clone, thiserror::Error)]
pub enum GpuError {
    /// No usable adapter (no GPU, no software rasteriser, or no compute shaders).
    #[error("no GPU adapter: {0}")]
    NoAdapter(String),
    /// The device could not be created or reported an error (validation, out of memory).
    #[error("GPU device error: {0}")]
    Device(String),
    /// The request is outside what the GPU paths implement.
    #[error("not supported on the GPU: {0}")]
    Unsupported(String),
    /// Reading results back failed.
    #[error("GPU readback failed: {0}")]
    Map(String),
    /// This deepfield was built without the `gpu` cargo feature (a headless build).
    #[error("this deepfield was built without the `gpu` feature (rebuild with default features for the GPU engines)")]
    NotBuilt,
}

/// How to install a software Vulkan rasteriser where there is no GPU.
pub const INSTALL_HINT: &str = "install a Vulkan driver; without a GPU, the software rasteriser lavapipe: \
     `apt-get install mesa-vulkan-drivers libvulkan1` (Debian/Ubuntu)";
