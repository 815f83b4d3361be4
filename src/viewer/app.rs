//! The explorer window: image, navigation, panels, progressive rendering, recolouring,
//! Julia preview, export and headless screenshots.
//!
//! The scene as edited lives in a `Document` (the scene file's formula, iteration limit
//! and layers, validated through the typed path, with the last valid [`Scene`]); the view in
//! `Navigation` (exact decimal centre and zoom, with its history). The scene shown is the
//! document's scene with the view's centre and zoom and the image area's size set through
//! the typed setters ([`Scene::with_view`], [`Scene::with_size`]); no TOML text is written
//! or read on the way. Whether that costs nothing, a recolour of the last raw planes
//! (milliseconds) or a render is decided by comparing typed values (`RenderState`). While
//! a new view renders, the last image is drawn where it belongs in the new view, so there is
//! never a blank frame.
//!
//! Split by concern: this file holds the app and its cycle (poll, request, draw) and the
//! saved session; the state lives in one struct per concern, each in its own file with
//! private fields (`document`, `navigation`, `render_state`, `julia_preview`,
//! `difference_view`, `screenshot`, `formula_chooser`); `panels` draws the toolbar, status
//! bar, controls and files in and out; `input` the keys and Newton zooming; `canvas` the
//! image area.
//!
//! The formula (any family of [`crate::formula::kind::KINDS`] or a hybrid) is chosen in the
//! side panel and named in the window title and status bar; the Julia preview and pick show
//! the Julia form of the formula shown. The GPU modes draw z² + c only: with another formula
//! the image is the CPU render.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use eframe::egui::{self, Color32, Key, PointerButton, Pos2, Rect, Sense, Vec2};

use super::export::{Export, ExportRequest};
use super::nav::Nav;
use super::palette_editor::PaletteEditor;
use super::worker::Worker;
use crate::formula::Formula;
use crate::orbit::saved::SavedReferences;
use crate::palette::{self, Palette};
use crate::scene::{Scene, SceneFile};
use difference_view::DifferenceView;
use document::Document;
use formula_chooser::FormulaChooser;
use input::NewtonState;
use julia_preview::JuliaPreview;
use navigation::Navigation;
use render_state::RenderState;
use screenshot::Screenshot;

mod canvas;
mod difference_view;
mod document;
mod formula_chooser;
mod input;
mod julia_preview;
mod navigation;
mod panels;
mod render_state;
mod screenshot;

/// How the image area shows the fractal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ViewMode {
    /// The CPU render (f64 or perturbation, as the engine choice says).
    Cpu,
    /// The GPU f32 shader, drawn by an egui paint callback.
    GpuF32,
    /// The GPU double-float shader.
    GpuDf,
    /// CPU left half, GPU (f32) right half.
    SideBySide,
    /// Per-pixel difference between the CPU image and the GPU image.
    Difference,
}

/// What the viewer starts with.
#[derive(Debug, Clone, Default)]
pub struct ViewerOptions {
    /// A scene file (TOML, .kfr, or a PNG/EXR written by deepfield).
    pub scene: Option<PathBuf>,
    /// Save a screenshot of the whole window here once the render is complete, then exit.
    pub screenshot: Option<PathBuf>,
    /// Render inline when polled (tests): no background thread.
    pub inline: bool,
    /// Reference orbits from a file (`deepfield reference`), used wherever they serve the
    /// view instead of computing them.
    pub references: Option<Arc<SavedReferences>>,
}

/// Counters a test (or the curious) can read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Passes rendered.
    pub renders: u64,
    /// Recolours from raw planes.
    pub recolours: u64,
    /// Julia previews rendered.
    pub julia_previews: u64,
    /// Deep engines built from the reference file's orbits.
    pub references_from_file: u64,
}

/// State saved between runs. Every field has a default, so a session saved by another
/// version (with fields added or gone) still opens: what it lacks takes the default.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(default)]
struct Saved {
    scene: String,
    nav: Nav,
    export_path: String,
    scene_path: String,
}

impl Default for Saved {
    fn default() -> Self {
        Saved {
            scene: "version = 1\n".into(),
            nav: Nav::home(),
            export_path: "deepfield-export.png".into(),
            scene_path: "scene.toml".into(),
        }
    }
}

/// The application.
pub struct ViewerApp {
    doc: Document,
    view: Navigation,
    render: RenderState,
    julia: JuliaPreview,
    diff: DifferenceView,
    export: Export,
    screenshot: Screenshot,
    newton: NewtonState,
    editor: PaletteEditor,
    chooser: FormulaChooser,
    /// The window title last set.
    title: String,
    /// How the image is shown.
    mode: ViewMode,
    /// Where "Save scene" writes.
    scene_path: String,
    /// The last problem to report in the status bar (a render that failed, a file that
    /// could not be opened or saved).
    error: Option<String>,
}

impl ViewerApp {
    /// A viewer on the scene of `options` (or the last session's, or the default).
    pub fn new(cc: &eframe::CreationContext<'_>, options: ViewerOptions) -> Result<Self, String> {
        let saved: Option<Saved> = cc.storage.and_then(|s| eframe::get_value(s, "deepfield"));
        let ctx = cc.egui_ctx.clone();
        let worker = if options.inline {
            Worker::inline(options.references.clone())
        } else {
            let c = ctx.clone();
            Worker::spawn(Arc::new(move || c.request_repaint()), options.references.clone())
        };
        let julia_worker = if options.inline {
            Worker::inline(None)
        } else {
            Worker::spawn(Arc::new(move || ctx.request_repaint()), None)
        };
        let default = || Document::from_text("default".into(), "version = 1\n", PathBuf::from("."));
        let (doc, saved_nav) = match (&options.scene, &saved) {
            (Some(path), _) => {
                let s = crate::io::read_scene_source(path).map_err(|e| e.to_string())?;
                (Document::from_text(s.origin, &s.text, s.base_dir).map_err(|e| e.to_string())?, None)
            }
            // A session that no longer validates (saved by another version) opens the default.
            (None, Some(saved)) => match Document::from_text("last session".into(), &saved.scene, PathBuf::from(".")) {
                Ok(doc) => (doc, Some(saved.nav.clone())),
                Err(_) => (default().map_err(|e| e.to_string())?, None),
            },
            (None, None) => (default().map_err(|e| e.to_string())?, None),
        };
        // A saved view keeps its centre and zoom; its rotation and stretch are the scene's.
        let scene_nav = Nav::of_scene(&doc.scene());
        let nav = saved_nav.map_or(scene_nav.clone(), |n| Nav { transform: scene_nav.transform, ..n });
        let mut app = Self {
            doc,
            view: Navigation::new(nav),
            render: RenderState::new(worker),
            julia: JuliaPreview::new(julia_worker),
            diff: DifferenceView::default(),
            export: Export::new(saved.as_ref().map(|s| s.export_path.clone())),
            screenshot: Screenshot::new(options.screenshot),
            newton: NewtonState::default(),
            editor: PaletteEditor::default(),
            chooser: FormulaChooser::default(),
            title: String::new(),
            mode: ViewMode::Cpu,
            scene_path: saved.as_ref().map_or_else(|| "scene.toml".into(), |s| s.scene_path.clone()),
            error: None,
        };
        // Deep views work in the viewer as in `render`; the GPU paint path needs a wgpu
        // render state (eframe's wgpu renderer provides it).
        if let Some(rs) = cc.wgpu_render_state.as_ref()
            && let Err(e) = crate::viewer::paint::register(rs)
        {
            app.error = Some(format!("GPU paint path unavailable: {e}"));
        }
        Ok(app)
    }

    /// The current view.
    pub fn nav(&self) -> &Nav {
        self.view.nav()
    }

    /// How the image is shown.
    pub fn mode(&self) -> ViewMode {
        self.mode
    }

    /// Shows the image as `mode` says (the GPU modes only for z² + c: with another formula
    /// the image stays the CPU render).
    pub fn set_mode(&mut self, mode: ViewMode) {
        self.mode = if self.doc.formula().is_quadratic() { mode } else { ViewMode::Cpu };
    }

    /// The formula shown.
    pub fn formula(&self) -> Formula {
        self.doc.formula()
    }

    /// The formula and its form, as the window title names them: `burning-ship^3 (Julia
    /// form)`.
    pub fn formula_title(&self) -> String {
        formula_chooser::formula_title(&self.doc.formula(), !self.doc.is_mandelbrot())
    }

    /// Makes the scene iterate `formula` in the form (Mandelbrot or Julia) it has, at the
    /// same view, and renders it; a formula the scene refuses changes nothing and says why.
    pub fn set_formula(&mut self, formula: Formula) -> Result<(), String> {
        if formula == self.doc.formula() {
            return Ok(());
        }
        self.doc.set_formula(formula).map_err(|e| e.message)?;
        if !formula.is_quadratic() {
            self.mode = ViewMode::Cpu;
        }
        self.render.invalidate();
        Ok(())
    }

    /// The whole set of the formula shown, in its form ([`Nav::default_for`]), with the
    /// view's rotation and stretch.
    pub fn default_view(&self) -> Nav {
        let transform = self.view.nav().transform;
        Nav { transform, ..Nav::default_for(&self.doc.formula(), !self.doc.is_mandelbrot()) }
    }

    /// The image area (points), as last laid out.
    pub fn image_rect(&self) -> Rect {
        self.view.image_rect()
    }

    /// The image area's size in physical pixels (the render size).
    pub fn image_size_px(&self) -> [u32; 2] {
        self.view.size_px()
    }

    /// Renders, recolours and previews done so far.
    pub fn counters(&self) -> Counters {
        let (renders, recolours, references_from_file) = self.render.counts();
        Counters { renders, recolours, julia_previews: self.julia.previews(), references_from_file }
    }

    /// The Julia parameter of the scene, if it is a Julia scene.
    pub fn julia_c(&self) -> Option<[String; 2]> {
        self.doc.julia_c()
    }

    /// The scene as edited so far (its view is [`ViewerApp::nav`]).
    pub fn scene_file(&self) -> &SceneFile {
        self.doc.file()
    }

    /// The palette of layer `k` (the editor's copy when it has one).
    pub fn layer_palette(&self, k: usize) -> Option<String> {
        self.doc.layer_palette(k)
    }

    /// Sets the palette of every layer that takes one (as `--palette` does).
    pub fn set_palette(&mut self, name: &str) {
        self.doc.set_palette(name);
        self.render.invalidate();
    }

    /// Opens the Julia set of `c` (decimal strings), the Julia form of the formula shown, as
    /// the main view.
    pub fn open_julia(&mut self, c: [String; 2]) {
        self.doc.set_julia(Some(c));
        let transform = self.view.nav().transform;
        self.go(Nav { center: ["0".into(), "0".into()], log10_zoom: 1.3f64.log10(), transform });
        self.render.invalidate();
    }

    /// Goes to `nav`, recording the current view in the history.
    pub fn go(&mut self, nav: Nav) {
        if self.view.go(nav) {
            self.render.invalidate();
        }
    }

    /// Back in the history.
    pub fn back(&mut self) {
        if self.view.back() {
            self.render.invalidate();
        }
    }

    /// Forward in the history.
    pub fn forward(&mut self) {
        if self.view.forward() {
            self.render.invalidate();
        }
    }

    /// The document's scene at the current view and the image area's size, through the
    /// typed setters.
    fn scene_for_view(&self) -> Result<Scene, String> {
        let nav = self.view.nav();
        let center = nav.center_decimal().map_err(|e| format!("view centre: {e}"))?;
        let scale = nav.scale().map_err(|e| format!("zoom: {e}"))?;
        let [w, h] = self.view.size_px();
        let scene = self.doc.scene();
        let aa = scene.aa;
        scene.with_view(center, scale).and_then(|s| s.with_size(w.max(1), h.max(1), aa)).map_err(|e| e.to_string())
    }

    /// Asks for the current view, when something changed since the last request.
    fn update_render(&mut self) {
        if !self.render.stale() || self.view.size_px()[0] == 0 {
            return;
        }
        match self.scene_for_view() {
            Ok(scene) => {
                self.error = None;
                let nav = self.view.nav().clone();
                self.render.request(scene, &nav);
            }
            Err(e) => {
                self.error = Some(e);
                // Asked again once something changes.
                self.render.request_failed();
            }
        }
    }

    fn poll(&mut self, ctx: &egui::Context) {
        if let Some(e) = self.render.poll(ctx) {
            self.error = Some(e);
        }
        if let Some(e) = self.diff.poll(ctx, self.mode == ViewMode::Difference, &self.render) {
            self.error = Some(e);
        }
        self.julia.poll(ctx);
    }

    /// The fraction of samples whose N differs between the CPU render and the GPU f32
    /// shader, once the difference mode has compared the current render.
    pub fn difference_mismatch(&self) -> Option<f64> {
        self.diff.shown_for(self.render.job()).map(|(_, m)| m)
    }

    /// Whether the last render is complete (no job in flight).
    pub fn idle(&self) -> bool {
        self.render.idle()
    }

    /// True once a requested screenshot was written (or failed: false).
    pub fn screenshot_written(&self) -> Option<bool> {
        self.screenshot.written()
    }
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.poll(&ctx);
        self.poll_newton(&ctx);
        self.dropped_files(&ctx);
        self.keys(&ctx);
        // The GPU modes draw z² + c only (a scene opened or chosen with another formula).
        if !self.doc.formula().is_quadratic() {
            self.mode = ViewMode::Cpu;
        }
        egui::Panel::top("toolbar").show(ui, |ui| self.toolbar(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        egui::Panel::left("controls").resizable(true).default_size(280.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.controls(ui));
        });
        egui::CentralPanel::default().show(ui, |ui| self.image_area(ui));
        let title = format!("deepfield — {}", self.formula_title());
        if title != self.title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
        self.update_render();
        self.julia.request(&self.doc);
        self.export.poll();
        if self.export.running() || !self.idle() {
            ctx.request_repaint();
        }
        let idle = self.idle();
        self.screenshot.step(&ctx, idle);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        let nav = self.view.nav();
        if let Some(scene) = self.doc.session_text(nav.center.clone(), nav.zoom_text()) {
            let saved = Saved {
                scene,
                nav: nav.clone(),
                export_path: self.export.path.clone(),
                scene_path: self.scene_path.clone(),
            };
            eframe::set_value(storage, "deepfield", &saved);
        }
    }
}

#[cfg(test)]
mod saved_tests {
    use super::*;

    /// A session saved with fields this version lacks, and without fields it has, opens.
    #[test]
    fn saved_sessions_survive_added_and_removed_fields() {
        let old = r#"{"scene": "version = 1\n", "nav": {"center": ["-1", "0"], "log10_zoom": 2.0}, "retired": 3}"#;
        let s: Saved = serde_json::from_str(old).expect("opens");
        assert_eq!(s.nav.center, ["-1", "0"]);
        assert_eq!(s.export_path, Saved::default().export_path);
    }
}
