//! Scenes built in code: a [`SceneFile`] put together by a program (the viewer, a test)
//! validated without source text, and setters that change one part of a validated
//! [`Scene`] (its view, size, Julia parameter, iteration limit) and check only that part.
//!
//! Validation locates its errors by the spans of the file's values. A file built in code has
//! no text for them to point into, so [`label`] numbers every value and keeps its key path
//! ("view.zoom", "layer[1].density"), and the same checks as for a file then report the key
//! path ([`SourceError::key`]) instead of a line and column. One set of checks serves files,
//! flags and code alike.

use std::path::Path;

use toml::Spanned;

use super::context::{BitmapLoadError, Ctx};
use super::raw::{KeyValueMut, LayerRaw, SceneFile, cli};
use super::validate::{self, View};
use super::{FamilySpec, Scene};
use crate::formula::Formula;
use crate::num::Decimal;
use crate::orbit::Scale;
use crate::source::SourceError;

/// The key path of key `key` of layer `k` (from 0), as errors from scenes built in code
/// name it.
pub fn layer_key(k: usize, key: &str) -> String {
    format!("layer[{k}].{key}")
}

impl Scene {
    /// Validates a scene file built in code. `origin` names it in errors, which carry the
    /// offending value's key path ([`SourceError::key`]) since there is no text to locate
    /// it in; `base_dir` resolves relative paths. The checks are those of
    /// [`Scene::validate`].
    pub fn from_file<E: Into<BitmapLoadError>>(
        file: SceneFile,
        origin: &str,
        base_dir: &Path,
        bitmaps: impl Fn(&Path) -> Result<crate::trap::Bitmap, E>,
    ) -> Result<Scene, SourceError> {
        let mut labelled = file.clone();
        let keys = label(&mut labelled);
        let load = |path: &Path| bitmaps(path).map_err(Into::into);
        let mut scene = validate::validate_in(labelled, &Ctx::keyed(origin, &keys), origin, base_dir, &load)?;
        // The scene keeps the file as built (its values' spans are not labels).
        let mut file = file;
        validate::anchor_paths(&mut file, base_dir);
        scene.file = file;
        Ok(scene)
    }

    /// The scene with its view centred on `center` at `scale` (rotation, stretch and
    /// projection kept). Only the view is checked again.
    pub fn with_view(mut self, center: [Decimal; 2], scale: Scale) -> Result<Scene, SourceError> {
        let mut file = self.file.clone();
        file.view.center = cli([center[0].text().to_string(), center[1].text().to_string()]);
        (file.view.zoom, file.view.radius) = match &scale {
            Scale::Zoom(z) => (Some(cli(z.text().to_string())), None),
            Scale::Radius(r) => (None, Some(cli(r.text().to_string()))),
        };
        let View { center, log10_radius, radius, scale, transform, projection } =
            self.check(&file, |cx, f| validate::view(cx, &f.view))?;
        self.file = file;
        (self.center, self.log10_radius, self.radius, self.scale) = (center, log10_radius, radius, scale);
        (self.transform, self.projection) = (transform, projection);
        Ok(self)
    }

    /// The scene at `width` x `height` pixels with `aa` x `aa` samples per pixel. Only the
    /// size is checked again.
    pub fn with_size(mut self, width: u32, height: u32, aa: u32) -> Result<Scene, SourceError> {
        let mut file = self.file.clone();
        file.view.width = cli(i64::from(width));
        file.view.height = cli(i64::from(height));
        file.render.aa = cli(i64::from(aa));
        (self.width, self.height, self.aa) = self.check(&file, |cx, f| validate::size(cx, &f.view, &f.render.aa))?;
        self.file = file;
        Ok(self)
    }

    /// The Julia form of the scene's formula at `c`, or its Mandelbrot form for None. Only
    /// the formula is checked again.
    pub fn with_julia(mut self, c: Option<[Decimal; 2]>) -> Result<Scene, SourceError> {
        let mut file = self.file.clone();
        if self.formula.is_quadratic() {
            // z² + c keeps the names its scenes have always had.
            file.formula.kind = cli(if c.is_some() { "julia" } else { "mandelbrot" }.to_string());
            file.formula.power = None;
        }
        file.formula.c = c.map(|c| cli([c[0].text().to_string(), c[1].text().to_string()]));
        (self.family, self.formula) = self.check(&file, |cx, f| validate::family(cx, &f.formula))?;
        self.file = file;
        Ok(self)
    }

    /// The scene iterating `formula`, in the form (Mandelbrot or Julia) it had. Only the
    /// formula is checked again.
    pub fn with_formula(mut self, formula: Formula) -> Result<Scene, SourceError> {
        let mut file = self.file.clone();
        let julia = file.formula.c.is_some();
        file.formula.kind =
            cli(if formula.is_quadratic() && julia { "julia".to_string() } else { formula.to_string() });
        file.formula.power = None;
        file.formula.a = formula.a().map(cli);
        (self.family, self.formula) = self.check(&file, |cx, f| validate::family(cx, &f.formula))?;
        self.file = file;
        Ok(self)
    }

    /// The scene iterating at most `max` times. Only the limit is checked again.
    pub fn with_max_iter(mut self, max: u32) -> Result<Scene, SourceError> {
        let mut file = self.file.clone();
        file.iteration.max = cli(i64::from(max));
        self.max_iter = self.check(&file, |cx, f| validate::max_iter(cx, &f.iteration.max))?;
        self.file = file;
        Ok(self)
    }

    /// The Julia parameter, for a Julia scene.
    pub fn julia_c(&self) -> Option<&[Decimal; 2]> {
        match &self.family {
            FamilySpec::Julia { c } => Some(c),
            FamilySpec::Mandelbrot => None,
        }
    }

    /// Runs one part of validation on `file` with errors that name key paths.
    fn check<T>(
        &self,
        file: &SceneFile,
        part: impl FnOnce(&Ctx<'_>, &SceneFile) -> Result<T, SourceError>,
    ) -> Result<T, SourceError> {
        let mut labelled = file.clone();
        let keys = label(&mut labelled);
        part(&Ctx::keyed(&self.origin, &keys), &labelled)
    }
}

/// Gives every value of `file` the span `k..k + 1`, `k` counting from 1, and returns the
/// key paths in that order: a value's span start `k` names `keys[k - 1]` ([`Ctx::keyed`]).
pub(super) fn label(file: &mut SceneFile) -> Vec<String> {
    let mut l = Labels::default();
    l.tag(&mut file.version, "version");
    l.tag(&mut file.formula.kind, "formula.kind");
    l.tag_opt(&mut file.formula.power, "formula.power");
    l.tag_opt(&mut file.formula.c, "formula.c");
    l.tag_opt(&mut file.formula.a, "formula.a");
    let v = &mut file.view;
    l.tag(&mut v.center, "view.center");
    l.tag_opt(&mut v.zoom, "view.zoom");
    l.tag_opt(&mut v.radius, "view.radius");
    l.tag(&mut v.width, "view.width");
    l.tag(&mut v.height, "view.height");
    l.tag_opt(&mut v.rotate, "view.rotate");
    l.tag_opt(&mut v.stretch_angle, "view.stretch_angle");
    l.tag_opt(&mut v.stretch_amount, "view.stretch_amount");
    l.tag_opt(&mut v.exponential_map, "view.exponential_map");
    l.tag(&mut file.iteration.max, "iteration.max");
    l.tag(&mut file.iteration.escape_radius, "iteration.escape_radius");
    let r = &mut file.render;
    l.tag(&mut r.aa, "render.aa");
    l.tag(&mut r.engine, "render.engine");
    l.tag_opt(&mut r.bla, "render.bla");
    l.tag_opt(&mut r.bla_tolerance, "render.bla_tolerance");
    l.tag_opt(&mut r.interior_detection, "render.interior_detection");
    l.tag_opt(&mut r.cycle, "render.cycle");
    l.tag(&mut r.background, "render.background");
    for (k, layer) in file.layers.iter_mut().enumerate() {
        l.tag(layer, format!("layer[{k}]"));
        l.layer(k, layer.get_mut());
    }
    l.tag_opt(&mut file.output.bits, "output.bits");
    l.tag_opt(&mut file.output.channels, "output.channels");
    l.keys
}

/// The key paths numbered so far.
#[derive(Default)]
struct Labels {
    keys: Vec<String>,
}

impl Labels {
    /// Numbers `v` as the value at `key`.
    fn tag<T: Clone>(&mut self, v: &mut Spanned<T>, key: impl Into<String>) {
        self.keys.push(key.into());
        let k = self.keys.len();
        *v = Spanned::new(k..k + 1, v.get_ref().clone());
    }

    /// Numbers `v`, where present.
    fn tag_opt<T: Clone>(&mut self, v: &mut Option<Spanned<T>>, key: impl Into<String>) {
        if let Some(v) = v {
            self.tag(v, key);
        }
    }

    /// Numbers every key of layer `k`, and those of its mask.
    fn layer(&mut self, k: usize, layer: &mut LayerRaw) {
        self.tag(&mut layer.kind, layer_key(k, "kind"));
        for (name, field) in layer.fields_mut() {
            let key = layer_key(k, name);
            match field {
                KeyValueMut::Number(v) => self.tag_opt(v, key),
                KeyValueMut::Integer(v) => self.tag_opt(v, key),
                KeyValueMut::Text(v) => self.tag_opt(v, key),
                KeyValueMut::Colors(v) => self.tag_opt(v, key),
                KeyValueMut::Point(v) => self.tag_opt(v, key),
                KeyValueMut::Triple(v) => self.tag_opt(v, key),
                KeyValueMut::Transfer(v) => self.tag_opt(v, key),
                KeyValueMut::Blend(v) => self.tag_opt(v, key),
                KeyValueMut::Mask(v) => {
                    if let Some(m) = v {
                        self.tag(m, key.clone());
                        let m = m.get_mut();
                        self.tag(&mut m.quantity, format!("{key}.quantity"));
                        self.tag_opt(&mut m.above, format!("{key}.above"));
                        self.tag_opt(&mut m.below, format!("{key}.below"));
                        self.tag_opt(&mut m.feather, format!("{key}.feather"));
                        self.tag_opt(&mut m.invert, format!("{key}.invert"));
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::raw::{FormulaRaw, IterationRaw, OutputRaw, RenderRaw, ViewRaw};

    const TEXT: &str = "version = 1\n[formula]\nkind = \"julia\"\nc = [\"-0.8\", \"0.156\"]\n[view]\n\
                        center = [\"0.1\", \"-0.2\"]\nzoom = \"3.5\"\nwidth = 64\nheight = 48\nrotate = 30.0\n\
                        [iteration]\nmax = 700\n[render]\naa = 2\n[[layer]]\nkind = \"smooth\"\npalette = \"fire\"\n\
                        density = 0.5\n[[layer]]\nkind = \"trap\"\nshape = \"circle\"\nradius = 0.25\n\
                        blend = \"multiply\"\n";

    fn parsed() -> Scene {
        let file = Scene::parse_file("text", TEXT).unwrap();
        Scene::validate(file, "text", TEXT, Path::new("."), crate::io::load_bitmap).unwrap()
    }

    fn layer(kind: &str, edit: impl FnOnce(&mut LayerRaw)) -> Spanned<LayerRaw> {
        let mut l = LayerRaw::of_kind(kind);
        edit(&mut l);
        cli(l)
    }

    /// The layers of [`TEXT`], built in code.
    fn layers() -> Vec<Spanned<LayerRaw>> {
        vec![
            layer("smooth", |l| {
                l.palette = Some(cli("fire".into()));
                l.density = Some(cli(0.5));
            }),
            layer("trap", |l| {
                l.shape = Some(cli("circle".into()));
                l.radius = Some(cli(0.25));
                l.blend = Some(cli(crate::compose::BlendMode::Multiply));
            }),
        ]
    }

    fn same_render(a: &Scene, b: &Scene) {
        assert_eq!(a.render_inputs(), b.render_inputs());
        assert_eq!(a.stack, b.stack);
        assert_eq!(a.traps, b.traps);
        assert_eq!((a.png_bits, a.channels), (b.png_bits, b.channels));
        assert!(a.planes_serve(b) && b.planes_serve(a));
    }

    fn d(t: &str) -> Decimal {
        Decimal::parse(t).unwrap()
    }

    /// A scene file built in code validates to the scene its TOML text does.
    #[test]
    fn a_file_built_in_code_is_the_scene_its_text_is() {
        let file = SceneFile {
            version: cli(1),
            formula: FormulaRaw {
                kind: cli("julia".into()),
                power: None,
                c: Some(cli(["-0.8".into(), "0.156".into()])),
                a: None,
            },
            view: ViewRaw {
                center: cli(["0.1".into(), "-0.2".into()]),
                zoom: Some(cli("3.5".into())),
                width: cli(64),
                height: cli(48),
                rotate: Some(cli(30.0)),
                ..ViewRaw::default()
            },
            iteration: IterationRaw { max: cli(700), ..IterationRaw::default() },
            render: RenderRaw { aa: cli(2), ..RenderRaw::default() },
            layers: layers(),
            output: OutputRaw::default(),
        };
        let built = Scene::from_file(file, "code", Path::new("."), crate::io::load_bitmap).unwrap();
        same_render(&built, &parsed());
        assert_eq!(built.to_toml(), parsed().to_toml(), "the same scene is embedded in outputs");
    }

    /// The setters reach the same scene from a plain Mandelbrot one, each checking its part.
    #[test]
    fn setters_change_one_part_each() {
        let view = ViewRaw { rotate: Some(cli(30.0)), ..ViewRaw::default() };
        let file = SceneFile {
            version: cli(1),
            formula: FormulaRaw::default(),
            view,
            iteration: IterationRaw::default(),
            render: RenderRaw::default(),
            layers: layers(),
            output: OutputRaw::default(),
        };
        let plain = Scene::from_file(file, "code", Path::new("."), crate::io::load_bitmap).unwrap();
        assert!(plain.julia_c().is_none());
        let scene = plain
            .clone()
            .with_julia(Some([d("-0.8"), d("0.156")]))
            .and_then(|s| s.with_view([d("0.1"), d("-0.2")], Scale::Zoom(d("3.5"))))
            .and_then(|s| s.with_size(64, 48, 2))
            .and_then(|s| s.with_max_iter(700))
            .unwrap();
        same_render(&scene, &parsed());
        assert_eq!(scene.julia_c(), Some(&[d("-0.8"), d("0.156")]));
        // The colouring is untouched, so the plain scene's planes would serve a recolour of
        // its own view, and not of another.
        assert_eq!(scene.stack, plain.stack);
        assert!(!plain.planes_serve(&scene));
        let moved = plain.clone().with_view([d("-0.75"), d("0")], Scale::Radius(d("1.25"))).unwrap();
        assert!(plain.planes_serve(&moved), "the same view, written the same way");
        let mut file = plain.file.clone();
        file.layers[0].get_mut().density = Some(cli(0.9));
        let recoloured = Scene::from_file(file, "code", Path::new("."), crate::io::load_bitmap).unwrap();
        assert_ne!(recoloured.stack, plain.stack);
        assert!(plain.planes_serve(&recoloured), "a colouring change only recolours");
    }

    /// A bad value built in code is refused with its key path, and so is one a setter is
    /// given.
    #[test]
    fn bad_values_built_in_code_name_their_key() {
        let mut file = Scene::parse_file("text", TEXT).unwrap();
        file.view.zoom = Some(cli("-3".into()));
        let e = Scene::from_file(file, "code", Path::new("."), crate::io::load_bitmap).unwrap_err();
        assert_eq!((e.key.as_deref(), e.position), (Some("view.zoom"), None), "{e}");
        assert_eq!(e.to_string(), "code: view.zoom: zoom must be positive, got -3");

        let mut file = Scene::parse_file("text", TEXT).unwrap();
        file.layers[1].get_mut().radius = Some(cli(f64::NAN));
        let e = Scene::from_file(file, "code", Path::new("."), crate::io::load_bitmap).unwrap_err();
        assert_eq!(e.key, Some(layer_key(1, "radius")), "{e}");

        let mut file = Scene::parse_file("text", TEXT).unwrap();
        file.layers[0].get_mut().mask = Some(cli(crate::scene::raw::MaskRaw::new("nowhere")));
        let e = Scene::from_file(file, "code", Path::new("."), crate::io::load_bitmap).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("layer[0].mask.quantity"), "{e}");

        let scene = parsed();
        let key = |r: Result<Scene, SourceError>| r.unwrap_err().key;
        assert_eq!(key(scene.clone().with_view([d("0"), d("0")], Scale::Zoom(d("0")))).as_deref(), Some("view.zoom"));
        assert_eq!(
            key(scene.clone().with_view([d("1e9"), d("0")], Scale::Zoom(d("1")))).as_deref(),
            Some("view.center")
        );
        assert_eq!(key(scene.clone().with_size(0, 10, 1)).as_deref(), Some("view.width"));
        assert_eq!(key(scene.clone().with_size(10, 10, 99)).as_deref(), Some("render.aa"));
        assert_eq!(key(scene.clone().with_max_iter(0)).as_deref(), Some("iteration.max"));
        assert_eq!(key(scene.with_julia(Some([d("0"), d("2e7")]))).as_deref(), Some("formula.c"));
    }

    /// Scenes from text keep their lines and columns.
    #[test]
    fn scenes_from_text_still_give_lines_and_columns() {
        let text = "version = 1\n[view]\nzoom = \"-1\"\n";
        let e =
            Scene::validate(Scene::parse_file("t", text).unwrap(), "t", text, Path::new("."), crate::io::load_bitmap)
                .unwrap_err();
        assert_eq!((e.key.clone(), e.to_string()), (None, "t:3:8: zoom must be positive, got -1".to_string()));
    }
}
