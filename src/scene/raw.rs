//! The scene file as written: serde structures that mirror the TOML one to one.
//!
//! Values that validation may reject are `Spanned`, so that an error points at the value's
//! line and column. Command-line overrides are written into this same structure with the
//! [`CLI`] span, so one validation path serves files and flags alike, and the structure
//! serialised back to TOML is the exact scene embedded in every PNG.

use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::coloring::Transfer;
use crate::compose::BlendMode;

/// Span marking a value that came from the command line rather than a file.
pub const CLI: std::ops::Range<usize> = usize::MAX..usize::MAX;

/// Wraps a command-line value.
pub fn cli<T>(value: T) -> Spanned<T> {
    Spanned::new(CLI, value)
}

/// A whole scene file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Format version; only 1 exists.
    pub version: Spanned<i64>,
    /// The map.
    #[serde(default)]
    pub formula: FormulaRaw,
    /// The window onto the plane.
    #[serde(default)]
    pub view: ViewRaw,
    /// Iteration limits.
    #[serde(default)]
    pub iteration: IterationRaw,
    /// Sampling and engine.
    #[serde(default)]
    pub render: RenderRaw,
    /// Colouring layers, bottom first.
    #[serde(default, rename = "layer", skip_serializing_if = "Vec::is_empty")]
    pub layers: Vec<Spanned<LayerRaw>>,
    /// Output settings.
    #[serde(default)]
    pub output: OutputRaw,
}

/// `[formula]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FormulaRaw {
    /// "mandelbrot" or "julia".
    pub kind: Spanned<String>,
    /// Julia parameter as decimal strings [re, im].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c: Option<Spanned<[String; 2]>>,
}

impl Default for FormulaRaw {
    fn default() -> Self {
        Self { kind: Spanned::new(0..0, "mandelbrot".into()), c: None }
    }
}

/// `[view]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ViewRaw {
    /// Centre as decimal strings [re, im].
    #[serde(default = "default_center")]
    pub center: Spanned<[String; 2]>,
    /// Zoom: the image height spans 4 / zoom.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zoom: Option<Spanned<String>>,
    /// Half the image height in the plane (= 2 / zoom).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<Spanned<String>>,
    /// Image width in pixels.
    #[serde(default = "default_width")]
    pub width: Spanned<i64>,
    /// Image height in pixels.
    #[serde(default = "default_height")]
    pub height: Spanned<i64>,
    /// Degrees the picture turns counter-clockwise (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate: Option<Spanned<f64>>,
    /// Direction of the stretch, degrees (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stretch_angle: Option<Spanned<f64>>,
    /// log2 of the stretch factor (default 0: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stretch_amount: Option<Spanned<f64>>,
}

impl ViewRaw {
    /// The rotation and stretch these keys describe (absent keys are 0; validation checks
    /// the ranges).
    pub fn transform(&self) -> crate::field::Transform {
        let v = |k: &Option<Spanned<f64>>| k.as_ref().map_or(0.0, |x| *x.get_ref());
        crate::field::Transform::new(v(&self.rotate), v(&self.stretch_angle), v(&self.stretch_amount))
    }
}

fn default_center() -> Spanned<[String; 2]> {
    Spanned::new(0..0, ["-0.75".into(), "0".into()])
}
fn default_width() -> Spanned<i64> {
    Spanned::new(0..0, 800)
}
fn default_height() -> Spanned<i64> {
    Spanned::new(0..0, 600)
}

impl Default for ViewRaw {
    fn default() -> Self {
        Self {
            center: default_center(),
            zoom: None,
            radius: None,
            width: default_width(),
            height: default_height(),
            rotate: None,
            stretch_angle: None,
            stretch_amount: None,
        }
    }
}

/// `[iteration]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct IterationRaw {
    /// Maximum iterations, 1 ..= 2^32 - 2.
    #[serde(default = "default_max")]
    pub max: Spanned<i64>,
    /// Escape radius R (>= 2).
    #[serde(default = "default_escape")]
    pub escape_radius: Spanned<f64>,
}

fn default_max() -> Spanned<i64> {
    Spanned::new(0..0, 1000)
}
fn default_escape() -> Spanned<f64> {
    Spanned::new(0..0, 65536.0)
}

impl Default for IterationRaw {
    fn default() -> Self {
        Self { max: default_max(), escape_radius: default_escape() }
    }
}

/// `[render]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RenderRaw {
    /// Supersampling factor N (N x N samples per pixel).
    #[serde(default = "default_aa")]
    pub aa: Spanned<i64>,
    /// "auto", "f64", "perturb-f64", "perturb-floatexp", "gpu" or "gpu-df".
    #[serde(default = "default_engine")]
    pub engine: Spanned<String>,
    /// Bilinear approximation in the perturbation engines (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bla: Option<Spanned<bool>>,
    /// BLA tolerance ε (default 1e-14).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bla_tolerance: Option<Spanned<f64>>,
    /// Interior detection in the perturbation engines (absent: where the view's centre is
    /// interior).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interior_detection: Option<Spanned<bool>>,
    /// Palette cycling: added to the offset of every palette, in cycles (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cycle: Option<Spanned<f64>>,
    /// Background colour below all layers, "#rrggbb".
    #[serde(default = "default_background")]
    pub background: Spanned<String>,
}

fn default_aa() -> Spanned<i64> {
    Spanned::new(0..0, 1)
}
fn default_engine() -> Spanned<String> {
    Spanned::new(0..0, "auto".into())
}
fn default_background() -> Spanned<String> {
    Spanned::new(0..0, "#000000".into())
}

impl Default for RenderRaw {
    fn default() -> Self {
        Self {
            aa: default_aa(),
            engine: default_engine(),
            bla: None,
            bla_tolerance: None,
            interior_detection: None,
            cycle: None,
            background: default_background(),
        }
    }
}

/// One `[[layer]]`: the union of every kind's keys; validation rejects keys that do not
/// apply to the layer's kind.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct LayerRaw {
    /// The colouring: see [`crate::scene::LAYER_KINDS`].
    pub kind: Spanned<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blend: Option<Spanned<BlendMode>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub opacity: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub palette: Option<Spanned<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transfer: Option<Spanned<Transfer>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interior: Option<Spanned<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub style: Option<Spanned<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<Spanned<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colors: Option<Spanned<[String; 2]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strength: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frequency: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<Spanned<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<Spanned<[f64; 2]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<Spanned<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threshold: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<Spanned<i64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<Spanned<i64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_width: Option<Spanned<i64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fold_offset: Option<Spanned<[f64; 3]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slice: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iterations: Option<Spanned<i64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<Spanned<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mask: Option<Spanned<MaskRaw>>,
}

impl Default for LayerRaw {
    fn default() -> Self {
        Self {
            kind: Spanned::new(0..0, String::new()),
            blend: None,
            opacity: None,
            palette: None,
            density: None,
            offset: None,
            transfer: None,
            interior: None,
            style: None,
            k: None,
            width: None,
            color: None,
            colors: None,
            height: None,
            strength: None,
            frequency: None,
            shape: None,
            center: None,
            angle: None,
            radius: None,
            image: None,
            size: None,
            threshold: None,
            frames: None,
            frame: None,
            frame_width: None,
            fold_offset: None,
            slice: None,
            iterations: None,
            decay: None,
            scale: None,
            mask: None,
        }
    }
}

/// `[layer.mask]`: where a layer applies.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaskRaw {
    /// "distance", "iteration", "phase" or "interior".
    pub quantity: Spanned<String>,
    /// Keep samples whose quantity is at least this.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub above: Option<Spanned<f64>>,
    /// Keep samples whose quantity is at most this.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub below: Option<Spanned<f64>>,
    /// Width of the soft edges.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feather: Option<Spanned<f64>>,
    /// Keep the complement.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub invert: Option<Spanned<bool>>,
}

/// `[output]`.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputRaw {
    /// PNG bit depth, 8 or 16.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bits: Option<Spanned<i64>>,
    /// EXR channels to write.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub channels: Option<Spanned<Vec<String>>>,
}

impl LayerRaw {
    /// A layer of the given kind with every option at its default.
    pub fn of_kind(kind: &str) -> Self {
        Self { kind: Spanned::new(0..0, kind.to_string()), ..Self::default() }
    }

    /// The keys present (other than `kind`), with their spans.
    pub fn present(&self) -> Vec<(&'static str, std::ops::Range<usize>)> {
        fn at<T>(v: &Option<Spanned<T>>) -> Option<std::ops::Range<usize>> {
            v.as_ref().map(|s| s.span())
        }
        let all = [
            ("blend", at(&self.blend)),
            ("opacity", at(&self.opacity)),
            ("palette", at(&self.palette)),
            ("density", at(&self.density)),
            ("offset", at(&self.offset)),
            ("transfer", at(&self.transfer)),
            ("interior", at(&self.interior)),
            ("style", at(&self.style)),
            ("k", at(&self.k)),
            ("width", at(&self.width)),
            ("color", at(&self.color)),
            ("colors", at(&self.colors)),
            ("height", at(&self.height)),
            ("strength", at(&self.strength)),
            ("frequency", at(&self.frequency)),
            ("shape", at(&self.shape)),
            ("center", at(&self.center)),
            ("angle", at(&self.angle)),
            ("radius", at(&self.radius)),
            ("image", at(&self.image)),
            ("size", at(&self.size)),
            ("threshold", at(&self.threshold)),
            ("frames", at(&self.frames)),
            ("frame", at(&self.frame)),
            ("frame_width", at(&self.frame_width)),
            ("fold_offset", at(&self.fold_offset)),
            ("slice", at(&self.slice)),
            ("iterations", at(&self.iterations)),
            ("decay", at(&self.decay)),
            ("scale", at(&self.scale)),
            ("mask", at(&self.mask)),
        ];
        all.into_iter().filter_map(|(k, s)| s.map(|s| (k, s))).collect()
    }
}
