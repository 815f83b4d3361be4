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
    /// A family's name ("mandelbrot", "burning-ship", ...), a hybrid (phases joined by
    /// `,`, each `NAME` or `NAME^P`), or "julia" (z² + c's Julia set).
    pub kind: Spanned<String>,
    /// The power of a single family (its smallest when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub power: Option<Spanned<i64>>,
    /// Julia parameter as decimal strings [re, im]: the formula's Julia form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c: Option<Spanned<[String; 2]>>,
    /// The coefficient a = [re, im] of the families that take one (Kalles Fraktaler's
    /// `FactorAR`, `FactorAI`; 1 when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<Spanned<[f64; 2]>>,
}

impl Default for FormulaRaw {
    fn default() -> Self {
        Self { kind: Spanned::new(0..0, "mandelbrot".into()), power: None, c: None, a: None }
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
    /// A strip of an exponential map covering radii `radius` down to `radius` / this
    /// factor, instead of a flat image (see `field::projection`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exponential_map: Option<Spanned<f64>>,
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
            exponential_map: None,
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

/// Declares the `[[layer]]` keys, each once, with its value type and the [`KeyValueMut`]
/// variant that views it, and generates from that one list everything that walks the keys:
/// the fields of [`LayerRaw`] (TOML names are the field names; absent keys are not written
/// back), its `Default`, [`LayerRaw::KEYS`], [`LayerRaw::present`] and
/// [`LayerRaw::fields_mut`]. The order of the list is the order keys are serialised in,
/// which the scenes embedded in existing outputs depend on. Which kinds take which key is
/// [`crate::scene::LAYER_KINDS`]'s table, and the value a kind uses for an absent key is
/// [`crate::scene::default_value`]'s.
macro_rules! layer_keys {
    ($($(#[doc = $doc:literal])+ $key:ident: $ty:ty => $view:ident,)+) => {
        /// One `[[layer]]`: the union of every kind's keys; validation rejects keys that do
        /// not apply to the layer's kind.
        #[derive(Debug, Clone, Deserialize, Serialize)]
        #[serde(deny_unknown_fields)]
        pub struct LayerRaw {
            /// The colouring: see [`crate::scene::LAYER_KINDS`].
            pub kind: Spanned<String>,
            $(
                $(#[doc = $doc])+
                #[serde(default, skip_serializing_if = "Option::is_none")]
                pub $key: Option<Spanned<$ty>>,
            )+
        }

        impl Default for LayerRaw {
            fn default() -> Self {
                Self { kind: Spanned::new(0..0, String::new()), $($key: None,)+ }
            }
        }

        impl LayerRaw {
            /// Every key a layer may have besides `kind`, in the order they are written.
            pub const KEYS: &'static [&'static str] = &[$(stringify!($key)),+];

            /// The keys present (other than `kind`), with their spans.
            pub fn present(&self) -> Vec<(&'static str, std::ops::Range<usize>)> {
                let mut keys = Vec::new();
                $(
                    if let Some(v) = &self.$key {
                        keys.push((stringify!($key), v.span()));
                    }
                )+
                keys
            }

            /// Every key besides `kind`, in [`LayerRaw::KEYS`] order, with a typed mutable view
            /// of its value (for editors: setting `Some` writes the key into the layer).
            pub fn fields_mut(&mut self) -> Vec<(&'static str, KeyValueMut<'_>)> {
                vec![$((stringify!($key), KeyValueMut::$view(&mut self.$key)),)+]
            }
        }
    };
}

layer_keys! {
    /// How the layer combines with those below it.
    blend: BlendMode => Blend,
    /// How much of the layer shows, 0 to 1.
    opacity: f64 => Number,
    /// A built-in palette's name or a palette file (relative to the scene file).
    palette: String => Text,
    /// Palette cycles per unit of the coloured quantity (the linear and log distance styles'
    /// scale).
    density: f64 => Number,
    /// Palette offset in cycles.
    offset: f64 => Number,
    /// Map from smooth iteration to palette position.
    transfer: Transfer => Transfer,
    /// Colour of the samples inside the set, "#rrggbb".
    interior: String => Text,
    /// Distance colouring: "soft", "linear" or "log".
    style: String => Text,
    /// Sharpness of the soft distance style.
    k: f64 => Number,
    /// Boundary line width in pixels.
    width: f64 => Number,
    /// A solid colour, "#rrggbb" (boundary lines, a solid interior).
    color: String => Text,
    /// The binary decomposition's two colours, "#rrggbb".
    colors: [String; 2] => Colors,
    /// Height of the slope light above the plane.
    height: f64 => Number,
    /// Strength of the slope light, or of the IFS field.
    strength: f64 => Number,
    /// Stripes per turn of the stripe average.
    frequency: f64 => Number,
    /// Trap shape: "point", "line", "cross" or "circle".
    shape: String => Text,
    /// Centre of a trap or bitmap in the plane.
    center: [f64; 2] => Point,
    /// Degrees: the slope light's direction, or a trap's or bitmap's rotation.
    angle: f64 => Number,
    /// Radius of a circle trap.
    radius: f64 => Number,
    /// The bitmap trap's PNG (relative to the scene file).
    image: String => Text,
    /// Size of the bitmap in the plane.
    size: f64 => Number,
    /// Alpha above which a bitmap sample stops the orbit.
    threshold: f64 => Number,
    /// Frames in a sprite-sheet bitmap.
    frames: i64 => Integer,
    /// The sprite-sheet frame shown, from 0.
    frame: i64 => Integer,
    /// Width of one sprite-sheet frame in texels.
    frame_width: i64 => Integer,
    /// The IFS field's fold offset (x, y, z).
    fold_offset: [f64; 3] => Triple,
    /// The IFS field's z slice.
    slice: f64 => Number,
    /// The IFS field's fold iterations.
    iterations: i64 => Integer,
    /// The IFS field's decay.
    decay: f64 => Number,
    /// The IFS field's scale.
    scale: f64 => Number,
    /// Where the layer applies.
    mask: MaskRaw => Mask,
}

/// A typed, mutable view of one layer key's value ([`LayerRaw::fields_mut`]): editors match
/// on the type instead of listing keys by hand.
#[derive(Debug)]
pub enum KeyValueMut<'a> {
    /// A number.
    Number(&'a mut Option<Spanned<f64>>),
    /// An integer.
    Integer(&'a mut Option<Spanned<i64>>),
    /// A word, a colour "#rrggbb", a palette or a path.
    Text(&'a mut Option<Spanned<String>>),
    /// Two colours.
    Colors(&'a mut Option<Spanned<[String; 2]>>),
    /// A point in the plane.
    Point(&'a mut Option<Spanned<[f64; 2]>>),
    /// Three numbers.
    Triple(&'a mut Option<Spanned<[f64; 3]>>),
    /// A transfer function.
    Transfer(&'a mut Option<Spanned<Transfer>>),
    /// A blend mode.
    Blend(&'a mut Option<Spanned<BlendMode>>),
    /// A mask table.
    Mask(&'a mut Option<Spanned<MaskRaw>>),
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

impl MaskRaw {
    /// A mask reading `quantity` over its whole range (every other key left out).
    pub fn new(quantity: &str) -> Self {
        MaskRaw { quantity: cli(quantity.to_string()), above: None, below: None, feather: None, invert: None }
    }
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Keys are written back in declaration order whatever order they were read in, absent
    /// keys are left out, and every declared key reads and writes under its own name.
    #[test]
    fn layer_keys_round_trip_in_declaration_order() {
        let text = "kind = \"ifs\"\nmask = { quantity = \"distance\", below = 8.0 }\nscale = 2.0\ndecay = 3.0\n\
                    iterations = 9\nslice = 0.5\nfold_offset = [1.0, 2.0, 3.0]\nframe_width = 4\nframe = 1\n\
                    frames = 2\nthreshold = 0.2\nsize = 1.5\nimage = \"a.png\"\nradius = 2.0\nangle = 30.0\n\
                    center = [0.5, -0.5]\nshape = \"circle\"\nfrequency = 4.0\nstrength = 0.5\nheight = 1.0\n\
                    colors = [\"#ffffff\", \"#000000\"]\ncolor = \"#ff0000\"\nwidth = 2.0\nk = 0.5\n\
                    style = \"log\"\ninterior = \"#00ff00\"\ntransfer = \"sqrt\"\noffset = 0.25\ndensity = 5000.0\n\
                    palette = \"fire\"\nopacity = 0.5\nblend = \"multiply\"\n";
        let mut l: LayerRaw = toml::from_str(text).unwrap();
        let present: Vec<&str> = l.present().into_iter().map(|(k, _)| k).collect();
        assert_eq!(present, LayerRaw::KEYS);
        let names: Vec<&str> = l.fields_mut().into_iter().map(|(k, _)| k).collect();
        assert_eq!(names, LayerRaw::KEYS);
        let expected = "kind = \"ifs\"\nblend = \"multiply\"\nopacity = 0.5\npalette = \"fire\"\ndensity = 5000.0\n\
                        offset = 0.25\ntransfer = \"sqrt\"\ninterior = \"#00ff00\"\nstyle = \"log\"\nk = 0.5\n\
                        width = 2.0\ncolor = \"#ff0000\"\ncolors = [\"#ffffff\", \"#000000\"]\nheight = 1.0\n\
                        strength = 0.5\nfrequency = 4.0\nshape = \"circle\"\ncenter = [0.5, -0.5]\nangle = 30.0\n\
                        radius = 2.0\nimage = \"a.png\"\nsize = 1.5\nthreshold = 0.2\nframes = 2\nframe = 1\n\
                        frame_width = 4\nfold_offset = [1.0, 2.0, 3.0]\nslice = 0.5\niterations = 9\ndecay = 3.0\n\
                        scale = 2.0\n\n[mask]\nquantity = \"distance\"\nbelow = 8.0\n";
        assert_eq!(toml::to_string(&l).unwrap(), expected);
        let only: LayerRaw = toml::from_str("kind = \"smooth\"\n").unwrap();
        assert!(only.present().is_empty());
        assert_eq!(toml::to_string(&only).unwrap(), "kind = \"smooth\"\n");
        assert!(toml::from_str::<LayerRaw>("kind = \"smooth\"\ndensty = 1.0\n").is_err(), "unknown keys are refused");
    }
}
