//! The scene being explored: the scene file as edited (formula and its Mandelbrot or Julia
//! form, iteration limit, layers), where it came from, the palette editor's palettes, and the
//! last valid typed [`Scene`].
//!
//! Every edit goes through [`Scene::from_file`], the typed path: no TOML text is written or
//! read; the formula and its form are what the typed setters [`Scene::with_formula`] and
//! [`Scene::with_julia`] make of them. An edit the scene refuses (a Julia parameter that is not a number, a colour that is
//! not "#rrggbb") leaves the last valid scene in place and keeps the error, whose key path
//! says which control to show it next to.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use toml::Spanned;

use crate::formula::Formula;
use crate::num::Decimal;
use crate::palette::Palette;
use crate::scene::raw::{FormulaRaw, LayerRaw, SceneFile, cli};
use crate::scene::{EngineChoice, Scene, uses_palette};
use crate::source::SourceError;

/// The scene file as edited and its last valid form.
pub(super) struct Document {
    file: SceneFile,
    origin: String,
    base_dir: PathBuf,
    /// The palette editor's palettes, by layer.
    overrides: BTreeMap<usize, Palette>,
    /// The layer the palette editor edits.
    selected_layer: usize,
    /// The file as last validated (at its own view and size).
    valid: Scene,
    /// Why the file as edited is not valid, while it is not.
    error: Option<SourceError>,
}

impl Document {
    /// Opens scene text: parsed and validated with errors located in `text` (a scene without
    /// layers gets a smooth one).
    pub(super) fn from_text(origin: String, text: &str, base_dir: PathBuf) -> Result<Self, SourceError> {
        let mut file = Scene::parse_file(&origin, text)?;
        if file.layers.is_empty() {
            file.layers.push(Spanned::new(0..0, LayerRaw::of_kind("smooth")));
        }
        let valid = Scene::validate(file.clone(), &origin, text, &base_dir, crate::io::load_bitmap)?;
        Ok(Self { file, origin, base_dir, overrides: BTreeMap::new(), selected_layer: 0, valid, error: None })
    }

    /// The scene file as edited.
    pub(super) fn file(&self) -> &SceneFile {
        &self.file
    }

    /// The last valid scene, with the palette editor's palettes in its layers.
    pub(super) fn scene(&self) -> Scene {
        let mut scene = self.valid.clone();
        for (k, p) in &self.overrides {
            if let Some(layer) = scene.stack.layers.get_mut(*k)
                && let Some(slot) = layer.coloring.palette_mut()
            {
                *slot = p.clone();
            }
        }
        scene
    }

    /// Why the file as edited is not valid.
    pub(super) fn error(&self) -> Option<&SourceError> {
        self.error.as_ref()
    }

    /// The error, when it is in the value at key path `key`.
    pub(super) fn error_at(&self, key: &str) -> Option<&SourceError> {
        self.error.as_ref().filter(|e| e.key.as_deref() == Some(key))
    }

    /// Validates the file as edited: it becomes the scene, or the error is kept and the last
    /// valid scene stays.
    fn revalidate(&mut self) {
        match Scene::from_file(self.file.clone(), &self.origin, &self.base_dir, crate::io::load_bitmap) {
            Ok(scene) => {
                self.valid = scene;
                self.error = None;
            }
            Err(e) => self.error = Some(e),
        }
    }

    /// The formula shown (the last valid scene's).
    pub(super) fn formula(&self) -> Formula {
        self.valid.formula
    }

    /// True for the Mandelbrot form of the formula (as edited): no Julia parameter.
    pub(super) fn is_mandelbrot(&self) -> bool {
        self.file.formula.c.is_none()
    }

    /// The Julia parameter as edited, for the Julia form of the formula.
    pub(super) fn julia_c(&self) -> Option<[String; 2]> {
        self.file.formula.c.as_ref().map(|c| c.get_ref().clone())
    }

    /// Makes the scene the Julia form of its formula at `c` (None: the Mandelbrot form).
    pub(super) fn set_julia(&mut self, c: Option<[String; 2]>) {
        self.file.formula = self.formula_form(c);
        self.revalidate();
    }

    /// Makes the scene iterate `formula`, in the form (Mandelbrot or Julia) it has, through
    /// [`Scene::with_formula`]; a formula it refuses leaves the scene as it is. The GPU
    /// engines draw z² + c only, so a scene set to one renders on the CPU ("auto")
    /// with any other formula.
    pub(super) fn set_formula(&mut self, formula: Formula) -> Result<(), SourceError> {
        let scene = self.valid.clone().with_formula(formula)?;
        self.file.formula.kind = scene.file.formula.kind;
        self.file.formula.power = scene.file.formula.power;
        if !formula.is_quadratic() && matches!(self.valid.engine, EngineChoice::Gpu | EngineChoice::GpuDf) {
            self.file.render.engine = cli("auto".into());
        }
        self.revalidate();
        Ok(())
    }

    /// The scene file's `[formula]` for the Julia form at `c` (None: the Mandelbrot form) of
    /// the formula shown, as [`Scene::with_julia`] writes it; `c` is kept as typed, and text
    /// that is not a number is left for validation to point at (`formula.c`).
    fn formula_form(&self, c: Option<[String; 2]>) -> FormulaRaw {
        let typed = match &c {
            None => Some(None),
            Some([re, im]) => Decimal::parse(re).and_then(|re| Ok(Some([re, Decimal::parse(im)?]))).ok(),
        };
        let mut raw = match typed.and_then(|c| self.valid.clone().with_julia(c).ok()) {
            Some(scene) => scene.file.formula,
            None => {
                let mut raw = self.file.formula.clone();
                if self.valid.formula.is_quadratic() {
                    raw.kind = cli(if c.is_some() { "julia" } else { "mandelbrot" }.into());
                    raw.power = None;
                }
                raw
            }
        };
        raw.c = c.map(cli);
        raw
    }

    /// The iteration limit as edited.
    pub(super) fn max_iter(&self) -> i64 {
        *self.file.iteration.max.get_ref()
    }

    /// Sets the iteration limit.
    pub(super) fn set_max_iter(&mut self, max: i64) {
        self.file.iteration.max = cli(max);
        self.revalidate();
    }

    /// The palette of layer `k` (the editor's copy when it has one).
    pub(super) fn layer_palette(&self, k: usize) -> Option<String> {
        self.overrides
            .get(&k)
            .map(|p| p.name.clone())
            .or_else(|| self.file.layers.get(k)?.get_ref().palette.as_ref().map(|p| p.get_ref().clone()))
    }

    /// Sets the palette of every layer that takes one (as `--palette` does).
    pub(super) fn set_palette(&mut self, name: &str) {
        for (k, l) in self.file.layers.iter_mut().enumerate() {
            let l = l.get_mut();
            if uses_palette(l) {
                l.palette = Some(cli(name.to_string()));
                self.overrides.remove(&k);
            }
        }
        self.revalidate();
    }

    /// The palette of the layer the editor edits, as the scene uses it.
    pub(super) fn selected_palette(&self) -> Option<Palette> {
        self.overrides
            .get(&self.selected_layer)
            .or_else(|| self.valid.stack.layers.get(self.selected_layer)?.coloring.palette())
            .cloned()
    }

    /// Gives the selected layer the palette `p` (the editor's, or a dropped file's).
    pub(super) fn override_selected(&mut self, p: Palette) {
        self.overrides.insert(self.selected_layer, p);
    }

    /// The layers panel; true when the scene changed.
    pub(super) fn layers_ui(&mut self, ui: &mut eframe::egui::Ui) -> bool {
        let changed = crate::viewer::layers_panel::show(
            ui,
            &mut self.file.layers,
            &mut self.overrides,
            &mut self.selected_layer,
            self.error.as_ref(),
        );
        if changed {
            self.revalidate();
        }
        changed
    }

    /// A Julia preview of `c` as a scene built in code: the Julia form of this scene's
    /// formula, its iteration limit (500 at most) and colouring, over the whole Julia set at
    /// 200 x 150 pixels.
    pub(super) fn julia_preview(&self, c: [f64; 2]) -> Result<Scene, SourceError> {
        let mut file = self.file.clone();
        file.formula = self.formula_form(Some([format!("{:.17e}", c[0]), format!("{:.17e}", c[1])]));
        file.view = Default::default();
        file.view.center = cli(["0".into(), "0".into()]);
        file.view.zoom = Some(cli("1.3".into()));
        file.view.width = cli(200);
        file.view.height = cli(150);
        file.render.aa = cli(1);
        file.render.engine = cli("auto".into());
        file.iteration.max = cli((*file.iteration.max.get_ref()).min(500));
        Scene::from_file(file, "julia preview", &self.base_dir, crate::io::load_bitmap)
    }

    /// Writes the scene to `path` at view `center`, `zoom` (decimal text); edited palettes
    /// are saved beside it and referred to by file name.
    pub(super) fn save(&self, path: &Path, center: [String; 2], zoom: String) -> Result<(), String> {
        let mut file = self.at_view(center, zoom);
        for (k, p) in &self.overrides {
            let stem = path.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
            let name = format!("{stem}-layer{k}.toml");
            let dir = path.parent().unwrap_or(Path::new("."));
            std::fs::write(dir.join(&name), crate::palette::to_toml(p)).map_err(|e| format!("{name}: {e}"))?;
            if let Some(l) = file.layers.get_mut(*k) {
                l.get_mut().palette = Some(cli(name));
            }
        }
        let text = toml::to_string(&file).map_err(|e| e.to_string())?;
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// The scene file at view `center`, `zoom`, as TOML (for the saved session).
    pub(super) fn session_text(&self, center: [String; 2], zoom: String) -> Option<String> {
        toml::to_string(&self.at_view(center, zoom)).ok()
    }

    /// The scene file as edited, at view `center`, `zoom`.
    fn at_view(&self, center: [String; 2], zoom: String) -> SceneFile {
        let mut file = self.file.clone();
        file.view.center = cli(center);
        file.view.zoom = Some(cli(zoom));
        file.view.radius = None;
        file
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::FamilySpec;

    fn doc(text: &str) -> Document {
        Document::from_text("test".into(), text, PathBuf::from(".")).expect("a valid scene")
    }

    fn formula(text: &str) -> Formula {
        Formula::parse(text, None).expect("a formula")
    }

    const VIEW: &str = "version = 1\n[view]\ncenter = [\"-0.5\", \"0.25\"]\nzoom = \"10\"\n[iteration]\nmax = 300\n";

    /// A family and power chosen: the scene iterates it, in its form, with the rest kept.
    #[test]
    fn a_formula_chosen_keeps_the_form_view_and_limit() {
        let mut d = doc(VIEW);
        d.set_formula(formula("burning-ship^3")).unwrap();
        let s = d.scene();
        assert_eq!(s.formula, formula("burning-ship^3"));
        assert!(d.is_mandelbrot() && matches!(s.family, FamilySpec::Mandelbrot));
        assert_eq!([s.center[0].text(), s.center[1].text()], ["-0.5", "0.25"]);
        assert_eq!((d.max_iter(), d.error().is_none()), (300, true));
        // A hybrid, then back to z² + c: the names z² + c's scenes have always had.
        d.set_formula(formula("burning-ship,mandelbrot^3")).unwrap();
        assert_eq!(d.file().formula.kind.get_ref(), "burning-ship,mandelbrot^3");
        d.set_formula(Formula::default()).unwrap();
        assert_eq!(d.file().formula.kind.get_ref(), "mandelbrot");
        assert!(d.scene().formula.is_quadratic());
    }

    /// The Julia pick and preview on a burning-ship scene are burning-ship Julia scenes;
    /// the Mandelbrot form again keeps the formula.
    #[test]
    fn julia_forms_keep_the_formula() {
        let ship = formula("burning-ship");
        let mut d = doc("version = 1\n[formula]\nkind = \"burning-ship\"\n");
        let preview = d.julia_preview([-0.5, 0.25]).expect("a preview");
        assert_eq!(preview.formula, ship);
        assert!(matches!(preview.family, FamilySpec::Julia { .. }));
        d.set_julia(Some(["-0.5".into(), "0.25".into()]));
        let s = d.scene();
        assert_eq!(s.formula, ship);
        assert_eq!(s.julia_c().map(|c| [c[0].text().to_string(), c[1].text().to_string()]), d.julia_c());
        assert_eq!(d.julia_c(), Some(["-0.5".to_string(), "0.25".to_string()]));
        // Text that is not a number is kept for its field, with the error at its key.
        d.set_julia(Some(["-0.5x".into(), "0.25".into()]));
        assert!(d.error_at("formula.c").is_some());
        assert_eq!(d.scene().formula, ship);
        d.set_julia(None);
        assert!(d.is_mandelbrot() && d.error().is_none());
        assert_eq!(d.scene().formula, ship);
        assert!(matches!(d.scene().family, FamilySpec::Mandelbrot));
        // z² + c's Julia form is still written `julia`, and its Mandelbrot form `mandelbrot`.
        let mut d = doc(VIEW);
        d.set_julia(Some(["-0.8".into(), "0.156".into()]));
        assert_eq!(d.file().formula.kind.get_ref(), "julia");
        d.set_formula(ship).unwrap();
        assert_eq!(d.file().formula.kind.get_ref(), "burning-ship");
        assert!(matches!(d.scene().family, FamilySpec::Julia { .. }));
        d.set_julia(None);
        assert_eq!(d.scene().formula, ship);
    }

    /// A scene set to a GPU engine renders another formula on the CPU.
    #[test]
    fn gpu_engines_give_way_for_other_formulas() {
        let mut d = doc("version = 1\n[render]\nengine = \"gpu\"\n");
        d.set_formula(formula("celtic^4")).unwrap();
        assert_eq!(d.scene().engine, EngineChoice::Auto);
        assert_eq!(d.scene().formula, formula("celtic^4"));
    }
}
